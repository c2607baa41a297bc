{{- define "uavtest.fullname" -}}
{{- printf "%s-operator" .Release.Name | trunc 63 | trimSuffix "-" -}}
{{- end -}}

{{- define "uavtest.labels" -}}
app.kubernetes.io/name: uavtest
app.kubernetes.io/instance: {{ .Release.Name }}
app.kubernetes.io/part-of: uavtest
app.kubernetes.io/managed-by: {{ .Release.Service }}
helm.sh/chart: {{ printf "%s-%s" .Chart.Name .Chart.Version }}
{{- end -}}

{{- define "uavtest.selector" -}}
app.kubernetes.io/name: uavtest
app.kubernetes.io/instance: {{ .Release.Name }}
app.kubernetes.io/component: operator
{{- end -}}

{{- define "uavtest.s3endpoint" -}}
{{- if .Values.store.endpoint -}}
{{ .Values.store.endpoint }}
{{- else if .Values.minio.enabled -}}
{{ printf "%s-minio.%s.svc:9000" .Release.Name .Release.Namespace }}
{{- else -}}
minio:9000
{{- end -}}
{{- end -}}
