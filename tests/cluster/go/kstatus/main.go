// kstatus reads Kubernetes objects as JSON (one object, or a List) on stdin and prints, for each,
// "<kind>/<name> <status> <message>" as sigs.k8s.io/cli-utils/pkg/kstatus computes it: the same
// library Flux (and kubectl-style "wait for Current") uses to decide whether an object is healthy.
package main

import (
	"encoding/json"
	"fmt"
	"io"
	"os"

	"k8s.io/apimachinery/pkg/apis/meta/v1/unstructured"
	"sigs.k8s.io/cli-utils/pkg/kstatus/status"
)

func main() {
	raw, err := io.ReadAll(os.Stdin)
	if err != nil {
		fmt.Fprintln(os.Stderr, "kstatus: reading stdin:", err)
		os.Exit(2)
	}
	// Unmarshal the Kubernetes way (integers stay int64, as kstatus' field accessors expect).
	var probe map[string]interface{}
	if err := json.Unmarshal(raw, &probe); err != nil {
		fmt.Fprintln(os.Stderr, "kstatus: not a JSON object:", err)
		os.Exit(2)
	}
	var items []*unstructured.Unstructured
	if _, isList := probe["items"]; isList {
		list := &unstructured.UnstructuredList{}
		if err := list.UnmarshalJSON(raw); err != nil {
			fmt.Fprintln(os.Stderr, "kstatus: not a list of objects:", err)
			os.Exit(2)
		}
		for i := range list.Items {
			items = append(items, &list.Items[i])
		}
	} else {
		u := &unstructured.Unstructured{}
		if err := u.UnmarshalJSON(raw); err != nil {
			fmt.Fprintln(os.Stderr, "kstatus: not an object:", err)
			os.Exit(2)
		}
		items = append(items, u)
	}
	for _, u := range items {
		res, err := status.Compute(u)
		if err != nil {
			fmt.Fprintf(os.Stderr, "kstatus: %s/%s: %v\n", u.GetKind(), u.GetName(), err)
			os.Exit(1)
		}
		fmt.Printf("%s/%s %s %s\n", u.GetKind(), u.GetName(), res.Status, res.Message)
	}
}
